//! `mint check` within a memory budget: the same [`CheckReport`] as the
//! in-core [`mint_mesh::check()`], for meshes of any size.
//!
//! The in-core check classifies every edge and fan from each vertex's own
//! incident faces. Here those incidences come from disk instead of a table
//! in memory:
//! 1. **positions**, one parallel pass: the bounding box, and the weld
//!    (unless `--no-weld`): positions go to buckets by a hash of their
//!    bits, each bucket's hashes go through a cache-sized table, and where
//!    hashes collide every vertex gets the smallest index at its position
//!    (`canonical`, kept only if something welds);
//! 2. **components**, a first pass over the faces: a union-find over
//!    vertices in face order (one thread) beside workers that sum per-face
//!    geometry in the in-core chunks (so volume and area are the same bits),
//!    and for each block of vertices the last chunk of faces touching it;
//! 3. **corners and vertices**, a second pass: each proper face goes once
//!    to the bucket of every vertex block it touches (one bucket when its
//!    vertices are near in number, as they mostly are: a third of the
//!    bytes of sending its three corners apart; collapsed faces' keys go
//!    to their own buckets), and a block is judged as soon as every chunk
//!    up to its last is done: its faces' corners `(v, a, b)` with `v` in
//!    the block are grouped by vertex (a counting sort) and each vertex is
//!    judged by
//!    [`mint_mesh::check::scan_vertex`], the in-core code itself. When faces
//!    and vertices run in a similar order, as in most files, corners are
//!    judged soon after they are made and never reach the disk; in any
//!    other order they spill and are judged at the end. A file without
//!    fixed-size records is read once, as a stream, for both passes.
//!
//! Memory: per vertex a union-find parent (4 bytes), two bits, and 4 more
//! bytes when welding merges anything; per component its Euler
//! characteristic; per simple boundary vertex one edge; nothing per face or
//! per edge beyond the buckets, which spill to disk past `--mem`. The
//! positions are read through the file's memory map and are not counted.
//! One vertex's incident faces must fit in memory.

use mint_core::progress::{Phase, Progress};
use mint_store::Budget;
use mint_io::{MeshReader, ReadOptions, TriangleChunk, VertexPositions};
use mint_mesh::check::{fan_pair, is_collapsed, report_from, scan_vertex, union_face, Bbox, FaceGeom, TopologyCounts, Totals, VertexScratch, FACE_CHUNK};
use mint_mesh::weld::position_key;
use mint_mesh::CheckReport;
use mint_store::{Buckets, Record, StoreError};
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::sync::Mutex;

/// Why a check failed; each text is one line naming the file.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    /// Reading the mesh failed (bad input).
    #[error(transparent)]
    Io(#[from] mint_io::Error),
    /// A spill bucket failed (full disk…).
    #[error(transparent)]
    Store(#[from] StoreError),
    /// A temporary directory or file failed.
    #[error("{path}: {op}: {source}")]
    Temp { path: PathBuf, op: &'static str, source: std::io::Error },
    /// The mesh is beyond what the check handles.
    #[error("{path}: {message}")]
    Limit { path: PathBuf, message: String },
    /// The user interrupted the check.
    #[error("interrupted")]
    Cancelled,
}

/// The outcome of one worker's chunk of faces: the visit's own error
/// first, then the sink's, then a pending Ctrl-C.
fn chunk_outcome(visited: Result<(), mint_io::Error>, sink: Option<StoreError>, progress: &dyn Progress) -> Option<CheckError> {
    match (visited, sink) {
        (Err(e), _) => Some(CheckError::from(e)),
        (_, Some(e)) => Some(e.into()),
        _ if progress.cancelled() => Some(CheckError::Cancelled),
        _ => None,
    }
}

/// Welding positions (units: vertices).
pub const WELD: Phase = Phase::named("check: weld");
/// First pass over the faces: components and geometry (units: faces).
pub const LINKS: Phase = Phase::named("check: components");
/// Second pass over the faces, judging vertices as they complete (units:
/// faces, then vertices).
pub const FACES: Phase = Phase::named("check: faces");
/// Judging the vertices of a streamed file (units: vertices).
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

/// A position's hash (the high half of the hash of its weld key; the low
/// bits chose its bucket) and its vertex. Equal positions have equal
/// hashes; equal hashes are then compared by position.
#[derive(Clone, Copy)]
struct Hashed {
    h: u32,
    v: u32,
}

impl Record for Hashed {
    const SIZE: usize = 8;
    #[inline]
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.h.to_le_bytes());
        out.extend_from_slice(&self.v.to_le_bytes());
    }
    #[inline]
    fn get(b: &[u8]) -> Self {
        Hashed { h: u32::from_le_bytes(b[..4].try_into().unwrap()), v: u32::from_le_bytes(b[4..8].try_into().unwrap()) }
    }
}

/// Three vertex indices: a proper face as written (welded), on its way to
/// the blocks of its vertices, or a collapsed face's sorted indices.
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
/// Checks the files of one surface (tiles) as one mesh: several files are
/// first written into one (f64 binary PLY in the spill directory, removed
/// at the end), so that welding joins their seams; one file is checked
/// as it is.
pub fn check_files(paths: &[PathBuf], opts: &CheckOptions, progress: &dyn Progress) -> Result<(CheckReport, CheckStats), CheckError> {
    if let [one] = paths {
        return check_file(one, opts, progress);
    }
    let tmp_root = opts.tmp_dir.clone().unwrap_or_else(std::env::temp_dir);
    let tmp = tempfile::Builder::new()
        .prefix(".mint-check-")
        .tempdir_in(&tmp_root)
        .map_err(|source| CheckError::Temp { path: tmp_root.clone(), op: "creating the check's spill directory", source })?;
    let joined = tmp.path().join("surface.ply");
    mint_io::concatenate(paths, &joined, mint_io::Format::Ply, mint_io::WriteOptions { ascii: false, double: true, spill_dir: Some(tmp.path().to_path_buf()), colours: false }, &|| progress.cancelled()).map_err(|e| if progress.cancelled() { CheckError::Cancelled } else { e.into() })?;
    check_file(&joined, opts, progress)
}

pub fn check_file(path: &Path, opts: &CheckOptions, progress: &dyn Progress) -> Result<(CheckReport, CheckStats), CheckError> {
    let tmp_root = opts.tmp_dir.clone().unwrap_or_else(std::env::temp_dir);
    let tmp = tempfile::Builder::new()
        .prefix(".mint-check-")
        .tempdir_in(&tmp_root)
        .map_err(|source| CheckError::Temp { path: tmp_root.clone(), op: "creating the check's spill directory", source })?;
    let dir = tmp.path();
    let mut reader = MeshReader::open(path, ReadOptions { chunk_triangles: FACE_CHUNK, spill_dir: Some(dir.to_path_buf()), resolve_positions: false })?;
    let positions = reader.positions();
    let nv = positions.len();
    // The check's shares of the budget (see `Budget::check`).
    let budget = Budget::new(opts.mem_bytes, opts.threads);
    let mut stats = CheckStats::default();

    let trace = std::env::var_os("MINT_CHECK_TRACE").is_some();
    let t0 = std::time::Instant::now();
    let lap = |what: &str| {
        if trace {
            eprintln!("check: {what} at {:.2}s", t0.elapsed().as_secs_f64());
        }
    };
    // 1. Bounding box over every position (welding never changes it), and
    // the weld.
    let (bbox, canonical, welded) = positions_pass(&positions, opts.weld, dir, &budget, opts.threads.max(1), progress, &mut stats)?;

    lap("weld");
    // 2. Faces, first pass: components, geometry, and for each block of
    // vertices the last chunk of faces that touches it.
    let threads = opts.threads.max(1);
    // Blocks of vertices: a power of two (a shift finds a vertex's block),
    // small enough that judging one stays in the caches, at most 4096.
    let block_shift = (nv as u64).div_ceil(4096).max(1 << 14).next_power_of_two().trailing_zeros();
    let block_vertices = 1u64 << block_shift;
    let blocks = (nv as u64).div_ceil(block_vertices).max(1);
    stats.vertex_blocks = blocks;
    let id = |v: u32| canonical.as_ref().map_or(v, |c: &Vec<u32>| c[v as usize]);
    // What is kept per vertex from here on: union-find parents, two bit
    // sets, the weld's map.
    let per_vertex = nv as u64 * 4 + nv as u64 / 4 + canonical.as_ref().map_or(0, |_| nv as u64 * 4);
    let (buckets, collapsed) = (budget.check_face_buckets(per_vertex), budget.check_collapsed_buckets(per_vertex));
    let sink = |n: usize, t: usize| Sink {
        by_block: Buckets::new(dir, &format!("faces-{t}"), blocks as usize, buckets / n as u64),
        collapsed: Buckets::new(dir, &format!("collapsed-{t}"), 64, collapsed / n as u64),
        block_shift,
    };
    let records = reader.triangle_records()?;
    let mut pass = None;
    if let Some(records) = &records {
        match links_direct(records, &id, &positions, threads, block_shift, blocks, progress) {
            Ok(p) => pass = Some((p, Vec::new())),
            // Polygons in a fixed-record file: read it as a stream.
            Err(CheckError::Io(e)) if e.kind() == mint_io::ErrorKind::Unsupported => {}
            Err(e) => return Err(e),
        }
    }
    let (links, sinks) = match pass {
        Some(p) => p,
        None => {
            let (links, filled) = faces_streamed(&mut reader, &id, &positions, blocks, sink(1, 0), progress)?;
            (links, vec![filled])
        }
    };
    let Links { mut parent, referenced, has_collapsed, geom, nfaces, last_chunk } = links;
    if nfaces > (u32::MAX / 3) as u64 {
        return Err(CheckError::Limit { path: path.to_path_buf(), message: format!("{nfaces} faces: `check` handles at most {} (u32 indices)", u32::MAX / 3) });
    }

    lap("links");
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

    // 3. Faces, second pass (fixed records only: the streamed pass above
    // already sent its faces), and vertices: each block judged as soon as
    // every chunk that touches it is done.
    let direct = sinks.is_empty();
    let sinks: Vec<Mutex<Sink>> = if direct { (0..threads).map(|t| Mutex::new(sink(threads, t))).collect() } else { sinks.into_iter().map(Mutex::new).collect() };
    let judged = corners_and_vertices(
        records.as_ref().filter(|_| direct),
        threads,
        &id,
        &sinks,
        &last_chunk,
        &Judge { labels: &labels, nv, block_vertices, list_boundary: opts.list_boundary, totals: Mutex::new((&mut chi, &mut bad)) },
        progress,
    )?;
    let (counts, mut simple, mut boundary) = judged;
    simple.sort_unstable();
    boundary.sort_unstable();
    boundary.truncate(opts.list_boundary);
    stats.boundary = boundary;

    lap("vertices");
    // Duplicates among collapsed faces: bucket b of every worker's set.
    let mut collapsed_sets = Vec::new();
    for s in sinks {
        let s = s.into_inner().unwrap();
        stats.bytes_spilled += s.by_block.bytes_spilled();
        collapsed_sets.push(s.collapsed.finish());
    }
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

/// Where one worker's proper faces (by vertex block) and collapsed faces go.
struct Sink {
    by_block: Buckets<Triple>,
    collapsed: Buckets<Triple>,
    /// A vertex's block is `v >> block_shift`.
    block_shift: u32,
}

impl Sink {
    /// One face (welded indices): to its vertex blocks, or its key if collapsed.
    #[inline]
    fn face(&mut self, f: [u32; 3]) -> Result<(), StoreError> {
        if is_collapsed(&f) {
            let mut k = f;
            k.sort_unstable();
            return self.collapsed.push((mix(&[k[0] as u64, k[1] as u64, k[2] as u64]) % 64) as usize, Triple(k));
        }
        // Once per block it touches (its corners in the block are
        // unpacked when the block is judged).
        let k = f.map(|v| (v >> self.block_shift) as usize);
        self.by_block.push(k[0], Triple(f))?;
        if k[1] != k[0] {
            self.by_block.push(k[1], Triple(f))?;
        }
        if k[2] != k[0] && k[2] != k[1] {
            self.by_block.push(k[2], Triple(f))?;
        }
        Ok(())
    }
}

/// What the first pass over the faces leaves.
struct Links {
    parent: Vec<u32>,
    referenced: Bits,
    has_collapsed: Bits,
    geom: FaceGeom,
    nfaces: u64,
    /// Per vertex block: the last chunk of [`FACE_CHUNK`] faces with a
    /// corner in it, or [`UNTOUCHED`].
    last_chunk: Vec<u32>,
}

/// Faces to look ahead when prefetching for vertices in no order.
const AHEAD: usize = 16;

/// Asks the CPU to start loading `parent[v]`.
#[inline(always)]
fn prefetch(parent: &[u32], v: u32) {
    #[cfg(target_arch = "x86_64")]
    if let Some(p) = parent.get(v as usize) {
        // SAFETY: a prefetch of a valid reference reads nothing and
        // cannot fault.
        unsafe { std::arch::x86_64::_mm_prefetch(p as *const u32 as *const i8, std::arch::x86_64::_MM_HINT_T0) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (parent, v);
}

/// A vertex block no face touches.
const UNTOUCHED: u32 = u32::MAX;

/// The union-find side of one face (welded indices).
#[inline]
fn link(parent: &mut [u32], referenced: &mut Bits, has_collapsed: &mut Bits, f: [u32; 3]) {
    for v in f {
        referenced.set(v);
    }
    union_face(parent, f);
    if is_collapsed(&f) {
        has_collapsed.set(f[0]);
    }
}

/// The first pass over a file with fixed-size records: one thread runs the
/// union-find over all faces in order and notes each vertex block's last
/// chunk, while workers sum the geometry of chunks of [`FACE_CHUNK`] faces
/// (combined in chunk order).
fn links_direct<I: Fn(u32) -> u32 + Sync>(
    records: &mint_io::TriangleRecords,
    id: &I,
    positions: &VertexPositions,
    threads: usize,
    block_shift: u32,
    blocks: u64,
    progress: &dyn Progress,
) -> Result<Links, CheckError> {
    let n = records.len();
    let nv = positions.len();
    let chunks = n.div_ceil(FACE_CHUNK as u64) as usize;
    let geoms: Mutex<Vec<FaceGeom>> = Mutex::new(vec![FaceGeom::default(); chunks]);
    let prefetch_corners = records.prefetch_pays(positions, (0, n));
    progress.start(LINKS, n);
    // The workers measure each chunk's geometry; beside them, this thread
    // links every face in order (the union-find is one sequential pass).
    let (failed, _, uf) = mint_core::pool::run(
        threads,
        chunks as u64,
        |_| Vec::<[u32; 3]>::with_capacity(FACE_CHUNK),
        |faces, c| {
            let (a, b) = (c * FACE_CHUNK as u64, ((c + 1) * FACE_CHUNK as u64).min(n));
            faces.clear();
            let visited = records.visit_indices(a, b, |_, t| faces.push(t.map(id)));
            let g = if visited.is_ok() { chunk_geometry(faces, positions, prefetch_corners) } else { FaceGeom::default() };
            if let Some(e) = chunk_outcome(visited, None, progress) {
                return Err(e);
            }
            geoms.lock().unwrap()[c as usize] = g;
            Ok(())
        },
        drop,
        |stop| {
            let uf = (|| -> Result<(Vec<u32>, Bits, Bits, Vec<u32>), CheckError> {
                let mut parent: Vec<u32> = (0..nv).collect();
                let mut referenced = Bits::new(nv as usize);
                let mut has_collapsed = Bits::new(nv as usize);
                let mut last_chunk = vec![UNTOUCHED; blocks as usize];
                let mut faces: Vec<[u32; 3]> = Vec::with_capacity(FACE_CHUNK);
                for c in 0..chunks {
                    let (a, b) = (c as u64 * FACE_CHUNK as u64, ((c + 1) as u64 * FACE_CHUNK as u64).min(n));
                    faces.clear();
                    records.visit_indices(a, b, |_, t| faces.push(t.map(id)))?;
                    for (k, &f) in faces.iter().enumerate() {
                        // Vertices in no order: start loading the parents of a
                        // face some way ahead.
                        if let Some(g) = faces.get(k + AHEAD) {
                            for &v in g {
                                prefetch(&parent, v);
                            }
                        }
                        link(&mut parent, &mut referenced, &mut has_collapsed, f);
                        for v in f {
                            last_chunk[(v >> block_shift) as usize] = c as u32;
                        }
                    }
                    progress.advance(b - a);
                    if stop.load(Ordering::Relaxed) {
                        break;
                    }
                    if progress.cancelled() {
                        return Err(CheckError::Cancelled);
                    }
                }
                Ok((parent, referenced, has_collapsed, last_chunk))
            })();
            if uf.is_err() {
                stop.store(true, Ordering::Relaxed);
            }
            uf
        },
    );
    if let Some(e) = failed {
        return Err(e);
    }
    let (parent, referenced, has_collapsed, last_chunk) = uf?;
    progress.finish();
    let geom = geoms.into_inner().unwrap().iter().fold(FaceGeom::default(), |acc, g| acc.then(g));
    Ok(Links { parent, referenced, has_collapsed, geom, nfaces: n, last_chunk })
}

/// The geometry sums of one chunk of faces (welded indices), at the
/// welded mesh's positions: each vertex's canonical one (-0.0 may have
/// become 0.0).
#[inline(never)]
fn chunk_geometry(faces: &[[u32; 3]], positions: &VertexPositions, prefetch: bool) -> FaceGeom {
    // Compiled for AVX2 as well, as resample's per-triangle loop is (see
    // `kernels::visit_chunk`): the same operations, fewer register copies.
    #[cfg(target_arch = "x86_64")]
    if mint_io::use_avx2() {
        #[target_feature(enable = "avx2")]
        unsafe fn with_avx2(faces: &[[u32; 3]], positions: &VertexPositions, prefetch: bool) -> FaceGeom {
            if prefetch {
                chunk_geometry_body::<true>(faces, positions)
            } else {
                chunk_geometry_body::<false>(faces, positions)
            }
        }
        // SAFETY: the CPU has AVX2 (checked by `use_avx2`).
        return unsafe { with_avx2(faces, positions, prefetch) };
    }
    if prefetch {
        chunk_geometry_body::<true>(faces, positions)
    } else {
        chunk_geometry_body::<false>(faces, positions)
    }
}

/// [`chunk_geometry`]'s work, inlined into each of its two compilations.
#[inline(always)]
fn chunk_geometry_body<const PREFETCH: bool>(faces: &[[u32; 3]], positions: &VertexPositions) -> FaceGeom {
    let mut g = FaceGeom::default();
    for (k, f) in faces.iter().enumerate() {
        // Only where locality is poor; see `TriangleRecords::prefetch_pays`.
        if !PREFETCH {
        } else if let Some(h) = faces.get(k + AHEAD) {
            for &v in h {
                positions.prefetch(v);
            }
        }
        // Three calls, not `f.map(..)`: the array map went through the
        // stack, and its stores and loads of mixed widths stalled.
        let (a, b, c) = (positions.get(f[0]), positions.get(f[1]), positions.get(f[2]));
        g.add(f, [a, b, c]);
    }
    g
}

/// The faces of any file, streamed in order by one thread: the first pass
/// and every corner (into `out`) at once.
fn faces_streamed(reader: &mut MeshReader, id: &dyn Fn(u32) -> u32, positions: &VertexPositions, blocks: u64, mut out: Sink, progress: &dyn Progress) -> Result<(Links, Sink), CheckError> {
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
            return Err(CheckError::Cancelled);
        }
    }
    if in_chunk > 0 {
        geom = geom.then(&g);
    }
    progress.finish();
    // Every block is ready once the stream is over.
    let last_chunk = vec![0; blocks as usize];
    Ok((Links { parent, referenced, has_collapsed, geom, nfaces, last_chunk }, out))
}

/// What judging a vertex block needs beside its corners.
struct Judge<'a> {
    labels: &'a [u32],
    nv: u32,
    block_vertices: u64,
    list_boundary: usize,
    /// Per component: Euler characteristic and "not closed".
    totals: Mutex<(&'a mut [i64], &'a mut [bool])>,
}

/// One worker's share of the judged vertices, and its buffers.
#[derive(Default)]
struct Judged {
    counts: TopologyCounts,
    /// Simple boundary vertices' outgoing edges (unsorted).
    simple: Vec<(u32, u32)>,
    /// Boundary edges, each worker's first `list_boundary` (unsorted).
    listed: Vec<[u32; 2]>,
    scratch: VertexScratch,
    start: Vec<u32>,
    fans: Vec<(u32, u32)>,
    records: Vec<Triple>,
    deltas: Vec<(u32, i64, bool)>,
}

impl Judge<'_> {
    /// Judges vertex block `blk`: takes its faces from every sink,
    /// groups their corners in the block by vertex (a counting sort) and scans each vertex; Euler
    /// characteristics and flags go to the vertex's component.
    fn block(&self, blk: u64, sinks: &[Mutex<Sink>], j: &mut Judged) -> Result<(), CheckError> {
        let v0 = (blk * self.block_vertices) as u32;
        let v1 = ((blk + 1) * self.block_vertices).min(self.nv as u64) as u32;
        let n = (v1 - v0) as usize;
        // The faces, in push order: the buckets' pages themselves when
        // none is on disk (the common case), else read into `records`.
        let buckets: Vec<mint_store::Bucket<Triple>> = sinks.iter().map(|sink| sink.lock().unwrap().by_block.take(blk as usize)).collect();
        let in_memory = buckets.iter().all(|b| b.pages().is_some());
        j.records.clear();
        let mut kept = Vec::new();
        if in_memory {
            kept = buckets;
        } else {
            for bucket in buckets {
                bucket.read(|batch| j.records.extend_from_slice(batch))?;
            }
        }
        let slices: Vec<&[Triple]> = if in_memory { kept.iter().flat_map(|b| b.pages().unwrap_or_default()).map(|p| &p[..]).collect() } else { vec![&j.records[..]] };
        if slices.iter().all(|s| s.is_empty()) {
            return Ok(());
        }
        // Counting sort of the faces' corners in the block, by vertex; a
        // vertex's fan keeps the faces' push order.
        j.start.clear();
        j.start.resize(n + 1, 0);
        let here = |v: u32| v.wrapping_sub(v0) < n as u32;
        for Triple(f) in slices.iter().copied().flatten() {
            for &v in f {
                if here(v) {
                    j.start[(v - v0) as usize + 1] += 1;
                }
            }
        }
        for i in 0..n {
            j.start[i + 1] += j.start[i];
        }
        j.fans.clear();
        j.fans.resize(j.start[n] as usize, (0, 0));
        let mut at = j.start.clone();
        for Triple(f) in slices.iter().copied().flatten() {
            for &v in f {
                if here(v) {
                    let s = &mut at[(v - v0) as usize];
                    j.fans[*s as usize] = fan_pair(f, v);
                    *s += 1;
                }
            }
        }
        drop(slices);
        drop(kept);
        j.deltas.clear();
        for i in 0..n {
            let (s, e) = (j.start[i] as usize, j.start[i + 1] as usize);
            if s == e {
                continue;
            }
            let v = v0 + i as u32;
            let t = scan_vertex(v, &j.fans[s..e], &mut j.scratch, &mut j.counts);
            j.deltas.push((self.labels[v as usize], t.faces_here as i64 - t.edges_here as i64, t.bad));
            if let Some(w) = t.simple_next {
                j.simple.push((v, w));
            }
            // Each worker keeps its smallest; the caller sorts and keeps
            // the smallest overall.
            if j.listed.len() < self.list_boundary {
                j.listed.extend(j.scratch.boundary_out.iter().map(|&w| [v, w]));
            }
        }
        let mut g = self.totals.lock().unwrap();
        for &(l, d, b) in &j.deltas {
            g.0[l as usize] += d;
            g.1[l as usize] |= b;
        }
        Ok(())
    }
}

/// The second pass's schedule: chunks of faces handed out in order, and
/// vertex blocks released for judging once every chunk that touches them
/// is done.
struct Schedule {
    next_chunk: usize,
    done: Vec<bool>,
    /// Chunks `0..prefix` are all done.
    prefix: usize,
    /// Touched blocks, by their last chunk.
    order: Vec<u32>,
    /// `order[..released]` may be judged; `order[..handed]` were handed out.
    released: usize,
    handed: usize,
    stop: bool,
}

enum Task {
    Chunk(usize),
    Block(u64),
}

/// The second pass over the faces and the judging of the vertices, on
/// `threads` workers. With `records`, the workers take chunks of faces in
/// order and send each proper face to their own sink (by vertex block), and a
/// block is judged as soon as the last chunk that touches it
/// (`last_chunk`) and every chunk before it are done: on a mesh whose
/// faces and vertices run in a similar order, faces are judged soon after
/// they are sent and never reach the disk. Judging comes before new
/// chunks. Without `records` the sinks are full already and every touched
/// block is judged. Returns the counts, simple boundary edges and listed
/// boundary edges, unsorted.
fn corners_and_vertices<I: Fn(u32) -> u32 + Sync>(
    records: Option<&mint_io::TriangleRecords>,
    threads: usize,
    id: &I,
    sinks: &[Mutex<Sink>],
    last_chunk: &[u32],
    judge: &Judge,
    progress: &dyn Progress,
) -> Result<(TopologyCounts, Vec<(u32, u32)>, Vec<[u32; 2]>), CheckError> {
    let n = records.map_or(0, |r| r.len());
    let chunks = n.div_ceil(FACE_CHUNK as u64) as usize;
    let mut order: Vec<u32> = (0..last_chunk.len() as u32).filter(|&b| last_chunk[b as usize] != UNTOUCHED).collect();
    order.sort_by_key(|&b| (last_chunk[b as usize], b));
    let released = if chunks == 0 { order.len() } else { 0 };
    let schedule = Mutex::new(Schedule { next_chunk: 0, done: vec![false; chunks], prefix: 0, order, released, handed: 0, stop: false });
    let wake = std::sync::Condvar::new();
    let failed: Mutex<Option<CheckError>> = Mutex::new(None);
    let fail = |e: CheckError| {
        failed.lock().unwrap().get_or_insert(e);
        schedule.lock().unwrap().stop = true;
        wake.notify_all();
    };
    progress.start(if chunks > 0 { FACES } else { VERTICES }, n + judge.nv as u64);
    let parts: Vec<Judged> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads)
            .map(|w| {
                let (schedule, wake, fail) = (&schedule, &wake, &fail);
                s.spawn(move || {
                    let mut j = Judged::default();
                    loop {
                        let task = {
                            let mut s = schedule.lock().unwrap();
                            loop {
                                if s.stop {
                                    return j;
                                }
                                if s.handed < s.released {
                                    s.handed += 1;
                                    break Task::Block(s.order[s.handed - 1] as u64);
                                }
                                if s.next_chunk < chunks {
                                    s.next_chunk += 1;
                                    break Task::Chunk(s.next_chunk - 1);
                                }
                                if s.handed == s.order.len() {
                                    return j;
                                }
                                s = wake.wait(s).unwrap();
                            }
                        };
                        match task {
                            Task::Chunk(c) => {
                                let records = records.expect("chunks only with records");
                                let (a, b) = (c as u64 * FACE_CHUNK as u64, ((c + 1) as u64 * FACE_CHUNK as u64).min(n));
                                let mut err = None;
                                let visited = {
                                    let mut out = sinks[w].lock().unwrap();
                                    records.visit_indices(a, b, |_, t| {
                                        if err.is_none() {
                                            err = out.face(t.map(id)).err();
                                        }
                                    })
                                };
                                if let Some(e) = chunk_outcome(visited, err, progress) {
                                    fail(e);
                                    return j;
                                }
                                progress.advance(b - a);
                                let mut s = schedule.lock().unwrap();
                                s.done[c] = true;
                                let mut released = false;
                                while s.prefix < chunks && s.done[s.prefix] {
                                    s.prefix += 1;
                                }
                                while s.released < s.order.len() && (last_chunk[s.order[s.released] as usize] as usize) < s.prefix {
                                    s.released += 1;
                                    released = true;
                                }
                                if released || s.next_chunk == chunks {
                                    wake.notify_all();
                                }
                            }
                            Task::Block(blk) => {
                                if let Err(e) = judge.block(blk, sinks, &mut j) {
                                    fail(e);
                                    return j;
                                }
                                let v1 = ((blk + 1) * judge.block_vertices).min(judge.nv as u64);
                                progress.advance(v1 - blk * judge.block_vertices);
                                if progress.cancelled() {
                                    fail(CheckError::Cancelled);
                                    return j;
                                }
                            }
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
    for j in parts {
        counts.add(&j.counts);
        simple.extend(j.simple);
        listed.extend(j.listed);
    }
    Ok((counts, simple, listed))
}

/// The pass over the positions: their bounding box (every finite one)
/// and, when `hash` (welding), each vertex's smallest index at its exact
/// position (finite positions only), or `None` when nothing welds, and how
/// many vertices were merged away. Workers take a share of the vertices
/// each (boxes merged: min and max do not depend on the split) and hash
/// positions into small buckets of `(hash, vertex)`; then each bucket's
/// hashes go into a table that fits the caches, and only vertices whose
/// hashes collide are compared by position.
fn positions_pass(positions: &VertexPositions, hash: bool, dir: &Path, budget: &Budget, threads: usize, progress: &dyn Progress, stats: &mut CheckStats) -> Result<(Bbox, Option<Vec<u32>>, u64), CheckError> {
    let nv = positions.len();
    // Buckets that each fit a sixteenth of the budget (a power of two, at
    // most 4096; few, so that spilling writes large pieces). The buckets
    // hold 5/8 of the budget, and each worker at most two buckets' worth.
    let nb = (nv as u64 * 8).div_ceil(budget.check_weld_bucket()).clamp(1, 4096).next_power_of_two() as usize;
    progress.start(WELD, nv as u64);
    let weld_share = budget.check_weld_per_thread();
    // Blocks of 2^20 vertices; each worker keeps its own box and buckets.
    const BLOCK: u32 = 1 << 20;
    let parts = mint_core::pool::collect(
        threads,
        nv.div_ceil(BLOCK) as u64,
        |t| (Bbox::empty(), Buckets::<Hashed>::new(dir, &format!("weld-{t}"), if hash { nb } else { 1 }, weld_share)),
        |(bbox, keyed), k| -> Result<(), StoreError> {
            let (v0, v1) = (k as u32 * BLOCK, (k as u32 * BLOCK).saturating_add(BLOCK).min(nv));
            for v in v0..v1 {
                let p = positions.get(v);
                bbox.add(p);
                if hash && p.iter().all(|c| c.is_finite()) {
                    let h = mix(&position_key(&p));
                    keyed.push(h as usize & (nb - 1), Hashed { h: (h >> 32) as u32, v })?;
                }
            }
            progress.advance((v1 - v0) as u64);
            Ok(())
        },
        |(bbox, keyed)| (bbox, keyed.finish()),
    )?;
    let mut bbox = Bbox::empty();
    let mut sets = Vec::new();
    for (b, set) in parts {
        bbox.merge(&b);
        stats.bytes_spilled += set.bytes_spilled();
        sets.push(Mutex::new(set));
    }
    progress.finish();
    if !hash {
        return Ok((bbox, None, 0));
    }
    // Each worker judges whole buckets with its own scratch, and keeps the
    // merges it found.
    #[derive(Default)]
    struct Scratch {
        merges: Vec<(u32, u32)>,
        recs: Vec<Hashed>,
        table: Vec<u32>,
        colliding: Vec<u32>,
        group: Vec<Hashed>,
        run: Vec<([u64; 3], u32)>,
        sorted: Vec<Hashed>,
        start: Vec<usize>,
    }
    let sets = &sets;
    let merges: Vec<Vec<(u32, u32)>> = mint_core::pool::collect(
        threads,
        nb as u64,
        |_| Scratch::default(),
        |w, b| -> Result<(), StoreError> {
            let b = b as usize;
            let Scratch { merges, recs, table, colliding, group, run, sorted, start } = w;
            recs.clear();
            for set in sets {
                let bucket = set.lock().unwrap().take(b);
                bucket.read(|batch| recs.extend_from_slice(batch))?;
            }
            // Split by 8 more bits of the hash (a counting
            // sort) into parts of a few thousand records, then
            // find the hashes seen twice in each part with an
            // open-addressing table of record numbers (+1) that
            // stays in the caches.
            let part = |h: u32| (h >> 8) as usize & 255;
            start.clear();
            start.resize(257, 0);
            for r in recs.iter() {
                start[part(r.h) + 1] += 1;
            }
            for i in 0..256 {
                start[i + 1] += start[i];
            }
            sorted.clear();
            sorted.resize(recs.len(), Hashed { h: 0, v: 0 });
            let mut at = start.clone();
            for r in recs.iter() {
                let k = &mut at[part(r.h)];
                sorted[*k] = *r;
                *k += 1;
            }
            for i in 0..256 {
                let these = &sorted[start[i]..start[i + 1]];
                let bits = (2 * these.len()).next_power_of_two().max(16).trailing_zeros();
                table.clear();
                table.resize(1 << bits, 0);
                colliding.clear();
                for (j, r) in these.iter().enumerate() {
                    let mut slot = (r.h.wrapping_mul(0x9E37_79B9) >> (32 - bits)) as usize;
                    loop {
                        let t = table[slot];
                        if t == 0 {
                            table[slot] = j as u32 + 1;
                            break;
                        }
                        if these[t as usize - 1].h == r.h {
                            colliding.push(r.h);
                            break;
                        }
                        slot = (slot + 1) & ((1 << bits) - 1);
                    }
                }
                if colliding.is_empty() {
                    continue;
                }
                // Equal hashes (in this part): compare the
                // positions themselves.
                colliding.sort_unstable();
                colliding.dedup();
                group.clear();
                group.extend(these.iter().filter(|r| colliding.binary_search(&r.h).is_ok()));
                group.sort_unstable_by_key(|r| (r.h, r.v));
                let mut g = 0;
                while g < group.len() {
                    let mut h = g + 1;
                    while h < group.len() && group[h].h == group[g].h {
                        h += 1;
                    }
                    run.clear();
                    run.extend(group[g..h].iter().map(|r| (position_key(&positions.get(r.v)), r.v)));
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
                    g = h;
                }
            }
            Ok(())
        },
        |w| w.merges,
    )?;
    let mut canonical: Option<Vec<u32>> = None;
    let mut merged = 0u64;
    for m in merges {
        for (v, c) in m {
            canonical.get_or_insert_with(|| (0..nv).collect())[v as usize] = c;
            merged += 1;
        }
    }
    Ok((bbox, canonical, merged))
}
