//! The streaming reader. [`MeshReader::open`] detects the format, maps the
//! file, and asks the format module for an `Opened`: the [`MeshInfo`], the
//! vertex `Positions` (memory-mapped, either in place or through a spill
//! file), an optional [`RangeGrid`], and a `FaceStream` that knows where
//! the faces are. [`MeshReader::next_chunk`] then pulls up to
//! [`ReadOptions::chunk_triangles`] triangles at a time into a
//! [`TriangleChunk`], through an `Emit` that range-checks indices and
//! resolves positions (rejecting NaN/infinite coordinates of used vertices).
//!
//! Memory: a reader holds the header, one chunk (which the caller owns and
//! reuses), and for range scans the grid; never anything per face, and
//! vertex positions only through maps. Spill files are anonymous temporary
//! files in `ReadOptions::spill_dir`, deleted when the reader is dropped.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::error::Error;
use crate::format::Format;
use crate::mapped::Mapped;
use crate::positions::{Emit, Positions};
pub use crate::backend::{ElementInfo, MeshInfo, RangeGrid, ReadStats};
use crate::backend::FaceStream;

/// Reads what the file says about itself without streaming its faces.
///
/// PLY, binary STL and OFF: header only; 3DS: the chunk headers. OBJ,
/// ascii STL, mesh, raw and VRML have no header with counts, so this scans
/// the whole file (one sequential pass over the mapped bytes, no spill) to
/// count vertices and faces.
pub fn read_info(path: &Path) -> Result<MeshInfo, Error> {
    let format = Format::from_path(path)?;
    let map = Mapped::open(path, &std::env::temp_dir())?;
    (crate::formats::backend(format).info)(path, map.bytes())
}

/// True when the file has per-vertex colour that [`MeshReader::colours`]
/// will give, or per-face colour ([`MeshReader::face_colours`]). Cheap for text OBJ (the first `v` line decides; the file is
/// mapped, not parsed); other formats open their header.
pub fn has_vertex_colour(path: &Path) -> Result<bool, Error> {
    match Format::from_path(path)? {
        Format::Obj => {
            let map = Mapped::open(path, &std::env::temp_dir())?;
            Ok(crate::obj::first_vertex_coloured(map.bytes()))
        }
        Format::Off | Format::Mesh | Format::Raw => Ok(false),
        _ => Ok(MeshReader::open(path, ReadOptions { chunk_triangles: 1, spill_dir: Some(std::env::temp_dir()), resolve_positions: false }).map(|r| r.colours().is_some() || r.face_colours().is_some() || r.texturing().is_some())?),
    }
}

/// Reads a whole mesh into memory: every vertex position and every
/// triangle (polygons fanned, strips unrolled, as the streaming reader
/// delivers them). For the in-core tools (simplify, contours, render's
/// reference); the out-of-core pipelines stream instead. A vertex used by a
/// face must be finite (the streaming reader's check). Nothing is reserved
/// from the header's counts, so a lying header costs nothing before it is
/// caught.
pub fn read_mesh(path: &Path) -> Result<(Vec<[f64; 3]>, Vec<[u32; 3]>), Error> {
    let whole = read_mesh_with(path, ReadOptions::default(), || true)?;
    Ok((whole.positions, whole.faces))
}

/// A mesh file's per-vertex colours as RGBA bytes by vertex index (alpha
/// 255 when the file has none), or `None` when it has no per-vertex colour.
/// Reads no face.
pub fn read_vertex_colours(path: &Path) -> Result<Option<Vec<[u8; 4]>>, Error> {
    let r = MeshReader::open(path, ReadOptions { chunk_triangles: 1, spill_dir: None, resolve_positions: false })?;
    Ok(r.colours().map(|c| (0..c.count()).map(|i| c.get(i)).collect()))
}

/// A whole mesh read by [`read_mesh_with`].
#[derive(Debug, Clone, Default)]
pub struct WholeMesh {
    /// Every vertex position, in file order.
    pub positions: Vec<[f64; 3]>,
    /// Every triangle (polygons fanned, strips unrolled).
    pub faces: Vec<[u32; 3]>,
    /// What the reader noticed (e.g. ignored trailing bytes), one line each.
    pub warnings: Vec<String>,
    /// False when `keep_going` asked to stop: the faces are then partial.
    pub complete: bool,
}

/// [`read_mesh`] with the reader's options (with `resolve_positions` off,
/// non-finite positions are read as they are, for tools that count them),
/// and `keep_going`, asked after every chunk of faces (false stops the
/// read: for Ctrl-C).
pub fn read_mesh_with(path: &Path, opts: ReadOptions, mut keep_going: impl FnMut() -> bool) -> Result<WholeMesh, Error> {
    let mut reader = MeshReader::open(path, opts)?;
    let positions: Vec<[f64; 3]> = (0..reader.vertex_count()).map(|i| reader.vertex(i)).collect();
    let mut faces = Vec::new();
    let mut chunk = TriangleChunk::new();
    while reader.next_chunk(&mut chunk)? {
        faces.extend_from_slice(&chunk.indices);
        if !keep_going() {
            return Ok(WholeMesh { positions, faces, warnings: reader.warnings(), complete: false });
        }
    }
    Ok(WholeMesh { positions, faces, warnings: reader.warnings(), complete: true })
}

/// Options of [`MeshReader::open`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReadOptions {
    /// Most triangles per [`MeshReader::next_chunk`]. Default 65536; 0 is
    /// treated as 1.
    pub chunk_triangles: usize,
    /// Where spill files (vertex positions of text files, ascii STL facets,
    /// inputs that cannot be mapped) go. Default `None`: the system
    /// temporary directory, [`std::env::temp_dir`]. Spill files are
    /// anonymous and vanish with the reader.
    pub spill_dir: Option<PathBuf>,
    /// Fill [`TriangleChunk::positions`] (and check that used vertices are
    /// finite). Default true; turn it off when only connectivity is needed.
    pub resolve_positions: bool,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions { chunk_triangles: 65536, spill_dir: None, resolve_positions: true }
    }
}

impl ReadOptions {
    pub(crate) fn spill_dir(&self) -> PathBuf {
        self.spill_dir.clone().unwrap_or_else(std::env::temp_dir)
    }
}

/// A batch of triangles. Reuse one chunk across calls: `next_chunk` clears
/// it and keeps its capacity.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct TriangleChunk {
    /// 0-based vertex indices of each triangle.
    pub indices: Vec<[u32; 3]>,
    /// The positions of the three corners (empty unless
    /// [`ReadOptions::resolve_positions`]).
    pub positions: Vec<[[f64; 3]; 3]>,
}

impl TriangleChunk {
    /// An empty chunk.
    pub fn new() -> TriangleChunk {
        TriangleChunk::default()
    }

    /// Triangles in the chunk.
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// True if the chunk holds no triangles.
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// Empties the chunk, keeping its capacity.
    pub fn clear(&mut self) {
        self.indices.clear();
        self.positions.clear();
    }
}

/// Vertex positions by index, shareable across threads; see
/// [`MeshReader::positions`]. Does not check for NaN (the reader checks
/// resolved triangles; callers resolving themselves check what they need).
#[derive(Debug, Clone)]
pub struct VertexPositions(Positions);

impl VertexPositions {
    /// Number of vertices.
    pub fn len(&self) -> u32 {
        self.0.count()
    }
    /// True when there are no vertices.
    pub fn is_empty(&self) -> bool {
        self.0.count() == 0
    }
    /// Position of vertex `i` (panics if `i >= len()`).
    #[inline(always)]
    pub fn get(&self, i: u32) -> [f64; 3] {
        self.0.get(i)
    }

    /// Asks the CPU to start loading vertex `i`'s position (a hint, for
    /// gathers in no spatial order; out-of-range indices are ignored).
    #[inline(always)]
    pub fn prefetch(&self, i: u32) {
        self.0.prefetch(i)
    }

    /// True when every coordinate is stored as `f32` or a narrower type, so
    /// that a copy kept as `f32` gives back the same `f64` values.
    pub fn exact_in_f32(&self) -> bool {
        self.0.exact_in_f32()
    }

    /// Bytes the positions span in their file (or spill), records whole.
    pub fn stored_bytes(&self) -> u64 {
        self.0.byte_range().1 as u64
    }

    /// Bytes from one vertex's record to the next (for locality estimates).
    pub fn stride(&self) -> u64 {
        (self.stored_bytes() / (self.len().max(1) as u64)).max(1)
    }

    /// The bounding box of vertices `first .. end` (clamped to `len()`),
    /// `Ok(None)` for an empty range, or `Err((i, p))` for the first vertex
    /// `i` whose position `p` is NaN or infinite. A tight loop for the
    /// common layouts (little-endian f32 or f64 records).
    pub fn bounds(&self, first: u32, end: u32) -> Result<Option<([f64; 3], [f64; 3])>, (u32, [f64; 3])> {
        use crate::positions::PosKind;
        let end = end.min(self.len());
        if first >= end {
            return Ok(None);
        }
        #[inline(always)]
        fn scan(first: u32, end: u32, get: impl Fn(u32) -> [f64; 3]) -> Result<Option<([f64; 3], [f64; 3])>, (u32, [f64; 3])> {
            let mut lo = [f64::INFINITY; 3];
            let mut hi = [f64::NEG_INFINITY; 3];
            for i in first..end {
                let p = get(i);
                if !(p[0] + p[1] + p[2]).is_finite() && !p.iter().all(|c| c.is_finite()) {
                    return Err((i, p));
                }
                for d in 0..3 {
                    lo[d] = lo[d].min(p[d]);
                    hi[d] = hi[d].max(p[d]);
                }
            }
            Ok(Some((lo, hi)))
        }
        if let Some(b) = self.0.packed_f32(first, end).and_then(packed_f32_bounds) {
            return Ok(Some(b));
        }
        match self.0.kind() {
            PosKind::F32Le => scan(first, end, |i| self.0.get_f32le(i)),
            PosKind::F64Le => scan(first, end, |i| self.0.get_f64le(i)),
            PosKind::Other => scan(first, end, |i| self.0.get_other(i)),
        }
    }
}

/// The bounding box of packed little-endian f32 triples, or `None` when a
/// coordinate is NaN or infinite (the caller then finds which, vertex by
/// vertex). Four vertices a step in twelve independent lanes, lane `i`
/// holding axis `i % 3`, which the compiler keeps in vector registers; the
/// scalar loop's `f64::min` per coordinate ran at a third of the speed.
/// f32 to f64 is exact and keeps order, so the box is the scalar loop's
/// (up to the sign of a zero bound, which no grid depends on).
fn packed_f32_bounds(bytes: &[u8]) -> Option<([f64; 3], [f64; 3])> {
    let mut lo = [f32::INFINITY; 12];
    let mut hi = [f32::NEG_INFINITY; 12];
    // `v - v` is 0 for a finite `v` and NaN otherwise; the sums stay 0
    // only if every coordinate is finite.
    let mut finite = [0.0f32; 12];
    let mut steps = bytes.chunks_exact(48);
    for s in &mut steps {
        for i in 0..12 {
            let v = f32::from_le_bytes([s[4 * i], s[4 * i + 1], s[4 * i + 2], s[4 * i + 3]]);
            lo[i] = if v < lo[i] { v } else { lo[i] };
            hi[i] = if v > hi[i] { v } else { hi[i] };
            finite[i] += v - v;
        }
    }
    for (k, s) in steps.remainder().chunks_exact(4).enumerate() {
        let v = f32::from_le_bytes([s[0], s[1], s[2], s[3]]);
        lo[k % 3] = if v < lo[k % 3] { v } else { lo[k % 3] };
        hi[k % 3] = if v > hi[k % 3] { v } else { hi[k % 3] };
        finite[k % 3] += v - v;
    }
    if finite.iter().any(|&f| f != 0.0) {
        return None;
    }
    let mut l = [f64::INFINITY; 3];
    let mut h = [f64::NEG_INFINITY; 3];
    for i in 0..12 {
        l[i % 3] = l[i % 3].min(lo[i] as f64);
        h[i % 3] = h[i % 3].max(hi[i] as f64);
    }
    Some((l, h))
}

/// The fewest bytes any format spends on one face record (binary PLY with
/// a `uchar` count and `uchar` indices: 4 bytes).
pub const MIN_FACE_RECORD_BYTES: u64 = 4;

/// `count` records of at least `min_record_bytes` bytes each, capped by what
/// `file_len` bytes can hold: the size to reserve for records a header
/// announces (the header may lie; the file's size does not).
pub fn capacity_hint(count: u64, file_len: u64, min_record_bytes: u64) -> usize {
    let cap = count.min(file_len / min_record_bytes.max(1));
    usize::try_from(cap).unwrap_or(usize::MAX)
}

/// A streaming mesh reader; see the module docs.
pub struct MeshReader {
    path: PathBuf,
    info: MeshInfo,
    positions: Positions,
    body: Box<dyn FaceStream>,
    range_grid: Option<RangeGrid>,
    colours: Option<crate::colours::VertexColours>,
    face_colours: Option<crate::colours::FaceColours>,
    texturing: Option<crate::textures::Texturing>,
    stats: ReadStats,
    opts: ReadOptions,
    bytes_total: u64,
    finished: bool,
}

impl std::fmt::Debug for MeshReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MeshReader")
            .field("path", &self.path)
            .field("info", &self.info)
            .field("stats", &self.stats)
            .field("finished", &self.finished)
            .finish_non_exhaustive()
    }
}

impl MeshReader {
    /// Opens `path` (format by extension, else sniffed), reads its header
    /// and makes vertex positions index-addressable. Text formats spill
    /// their positions here (one pass over the vertex data).
    pub fn open(path: &Path, opts: ReadOptions) -> Result<MeshReader, Error> {
        let format = Format::from_path(path)?;
        let spill_dir = opts.spill_dir();
        let map = Arc::new(Mapped::open(path, &spill_dir)?);
        let bytes_total = map.bytes().len() as u64;
        let opened = (crate::formats::backend(format).open)(path, map, &spill_dir)?;
        Ok(MeshReader {
            path: path.to_path_buf(),
            info: opened.info,
            positions: opened.positions,
            body: opened.body,
            range_grid: opened.range_grid,
            colours: opened.colours,
            face_colours: opened.face_colours,
            texturing: opened.texturing,
            stats: ReadStats { spilled_vertices: opened.spilled_vertices, ..ReadStats::default() },
            opts,
            bytes_total,
            finished: false,
        })
    }

    /// Opens `path` to read only its face records `first .. end`, for
    /// splitting one file's faces among independent workers. The file must
    /// be splittable (see [`MeshReader::splittable_records`]); every record
    /// in the range must be a triangle, or reading fails naming the record.
    /// Chunks hold [`ReadOptions::chunk_triangles`] triangles counted from
    /// `first`.
    pub fn open_range(path: &Path, opts: ReadOptions, first: u64, end: u64) -> Result<MeshReader, Error> {
        let mut r = MeshReader::open(path, opts)?;
        match r.body.splittable_records() {
            Some(n) if first <= end && end <= n => r.body.restrict(first, end)?,
            Some(n) => {
                return Err(Error::unsupported(path, format!("face records {first}..{end} asked of a file with {n}")));
            }
            None => {
                return Err(Error::unsupported(
                    path,
                    "this file's faces cannot be read in parts (only binary PLY with one face element and binary STL can); convert it with `mint convert IN OUT.ply`",
                ));
            }
        }
        Ok(r)
    }

    /// The number of face records when the file's faces can be read in
    /// independent ranges with [`MeshReader::open_range`] (binary PLY with
    /// one face element whose other properties are fixed-size, binary STL),
    /// else `None`.
    pub fn splittable_records(&self) -> Option<u64> {
        self.body.splittable_records()
    }

    /// A thread-safe handle that visits any range of this file's face
    /// records directly from the map, with positions resolved, when the
    /// file's records have one size (see [`MeshReader::splittable_records`]);
    /// `None` otherwise. Several threads can visit disjoint ranges at once.
    pub fn triangle_records(&self) -> Result<Option<crate::visit::TriangleRecords>, Error> {
        Ok(self.body.fixed_faces()?.map(|f| crate::visit::TriangleRecords::new(self.path.clone(), self.positions.clone(), f)))
    }

    /// The file this reader reads.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// What the header says.
    pub fn info(&self) -> &MeshInfo {
        &self.info
    }

    /// How many triangles to reserve room for before reading the faces:
    /// the header's face count, capped by what the file can hold (every
    /// face record takes at least [`MIN_FACE_RECORD_BYTES`] bytes, and a
    /// strip or polygon at least one more byte per extra triangle), so a
    /// header that lies about its counts cannot make a loader ask for more
    /// memory than the file's size; the truncation is then reported by
    /// [`MeshReader::next_chunk`] as for any short file.
    pub fn face_capacity_hint(&self) -> usize {
        capacity_hint(self.info.face_count.unwrap_or(0), self.bytes_total, MIN_FACE_RECORD_BYTES)
    }

    /// Per-vertex colour, when the file has it (PLY `red green blue
    /// [alpha]`, OBJ `v x y z r g b`); RGBA bytes by vertex index.
    pub fn colours(&self) -> Option<crate::colours::VertexColours> {
        self.colours.clone()
    }

    /// Per-face colour (PLY faces with `red green blue [alpha]`), by
    /// triangle: triangle `t` of the whole file's stream (a polygon of n
    /// corners gives n − 2 triangles, in order; a reader opened on records
    /// `first ..` of a split file starts at triangle `first`). `None` when
    /// the file has none, or has per-vertex colour ([`MeshReader::colours`]
    /// wins).
    pub fn face_colours(&self) -> Option<crate::colours::FaceColours> {
        self.face_colours.clone()
    }

    /// Texture coordinates and materials (OBJ with `mtllib` and `vt`; glTF
    /// with `baseColorTexture`), by triangle as [`MeshReader::face_colours`].
    /// `None` when the file has none, or has per-vertex colour.
    pub fn texturing(&self) -> Option<crate::textures::Texturing> {
        self.texturing.clone()
    }

    /// Number of vertices (for STL: 3 per facet).
    pub fn vertex_count(&self) -> u32 {
        self.positions.count()
    }

    /// Position of vertex `i`, read from the map (no finiteness check).
    /// Panics if `i >= vertex_count()`.
    pub fn vertex(&self, i: u32) -> [f64; 3] {
        self.positions.get(i)
    }

    /// A cheap, thread-safe handle on the vertex positions (it shares the
    /// reader's memory map), so worker threads can resolve indices that the
    /// reader streams with `resolve_positions: false`.
    pub fn positions(&self) -> VertexPositions {
        VertexPositions(self.positions.clone())
    }

    /// Clears `chunk` and fills it with up to
    /// [`ReadOptions::chunk_triangles`] triangles. Returns `Ok(false)` (and
    /// an empty chunk) when no triangles remain. After an error the reader
    /// is finished and the chunk's content is unspecified.
    pub fn next_chunk(&mut self, chunk: &mut TriangleChunk) -> Result<bool, Error> {
        chunk.clear();
        if self.finished {
            return Ok(false);
        }
        let max = self.opts.chunk_triangles.max(1);
        let resolve = self.opts.resolve_positions;
        chunk.indices.reserve(max.min(1 << 22));
        if resolve {
            chunk.positions.reserve(max.min(1 << 22));
        }
        let mut out = Emit { indices: &mut chunk.indices, positions: &mut chunk.positions, max, resolve, pos: &self.positions };
        match self.body.fill(&mut out, &mut self.stats) {
            Ok(more) => self.finished = !more,
            Err(e) => {
                self.finished = true;
                return Err(e);
            }
        }
        self.stats.triangles += chunk.len() as u64;
        Ok(!chunk.is_empty())
    }

    /// Size of the input in bytes, for progress bars.
    pub fn bytes_total(&self) -> u64 {
        self.bytes_total
    }

    /// Bytes of the input consumed so far (equals [`bytes_total`] when all
    /// faces have been read).
    ///
    /// [`bytes_total`]: MeshReader::bytes_total
    pub fn bytes_done(&self) -> u64 {
        if self.finished {
            self.bytes_total
        } else {
            self.body.bytes_done().min(self.bytes_total)
        }
    }

    /// The range grid of a PLY range scan (`range_grid` element with
    /// `obj_info num_cols`/`num_rows`), or `None`. Parsed at `open`; this
    /// returns a copy (8 bytes per cell).
    pub fn range_grid(&self) -> Option<RangeGrid> {
        self.range_grid.clone()
    }

    /// Counters so far: triangles, skipped short faces, dropped degenerate
    /// strip triangles, spilled vertices.
    pub fn stats(&self) -> ReadStats {
        ReadStats { ignored_trailing_bytes: self.body.ignored_trailing_bytes(), ..self.stats }
    }

    /// What the reader accepted but a user should know, one line each,
    /// naming the file (so far; complete once every face has been read).
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        let n = self.body.ignored_trailing_bytes();
        if n > 0 {
            w.push(format!("{}: {n} bytes after the last element the header declares were ignored (the header counts may not match the body)", self.path.display()));
        }
        w.extend(self.body.warnings());
        if let Some(t) = &self.texturing {
            w.extend(t.warnings.iter().cloned());
        }
        w
    }
}

/// Positions this small are not prefetched (they stay in the caches).
pub const PREFETCH_CACHE_BYTES: u64 = 8 << 20;

/// Sampled locality: windows of this many consecutive faces…
const WINDOW: u64 = 1024;
/// …this many of them, spread over the faces.
const WINDOWS: u64 = 64;
/// Above this many pages per face (sampled), visiting should prefetch.
/// Measured on a 20M-face torus with its vertices shuffled within windows
/// (resample to 3M cells, warm): in order (0.005) prefetching cost 15-25%
/// of user time; windows of 3,000 vertices (0.016) were a tie; 30,000
/// (0.09) and 300,000 (0.59) gained 10-20% from it.
pub const PREFETCH_PAGES_PER_FACE: f64 = 0.01;

/// Sampling the locality of a mesh's faces (which decides prefetching,
/// and `--deref auto`).
impl crate::visit::TriangleRecords {
    /// Whether visiting records `range` should prefetch corners ahead
    /// ([`TriangleRecords::set_prefetch`]): when a sample of the faces touches
    /// more than [`PREFETCH_PAGES_PER_FACE`] pages of positions per face.
    /// Below that, neighbouring faces share pages, the hardware prefetcher
    /// follows them, and the look-ahead only costs (a fifth of the visit on a
    /// generated torus in order). Which one runs does not change any result.
    /// Positions of at most [`PREFETCH_CACHE_BYTES`] stay in the cache
    /// whatever the order: no prefetching, and no sample (which a tile of
    /// a few hundred thousand faces would pay 64 times over).
    pub fn prefetch_pays(&self, positions: &VertexPositions, range: (u64, u64)) -> bool {
        positions.stored_bytes() > PREFETCH_CACHE_BYTES && self.pages_per_face(positions, range) > PREFETCH_PAGES_PER_FACE
    }

    /// Distinct 4 KiB pages of positions touched per face, over [`WINDOWS`]
    /// windows of [`WINDOW`] consecutive faces spread evenly over `range`.
    pub fn pages_per_face(&self, positions: &VertexPositions, (first, end): (u64, u64)) -> f64 {
        let records = self;
        let end = end.min(records.len());
        let n = end.saturating_sub(first);
        if n == 0 {
            return 0.0;
        }
        let stride = positions.stride();
        let (mut pages, mut faces) = (0u64, 0u64);
        let mut ids: Vec<u64> = Vec::with_capacity(3 * WINDOW as usize);
        for w in 0..WINDOWS.min(n.div_ceil(WINDOW)) {
            let a = first + n.saturating_sub(WINDOW) * w / WINDOWS.max(1);
            let b = (a + WINDOW).min(end);
            ids.clear();
            // A bad record is reported by the pass itself; a sample ignores it.
            let _ = records.visit_indices(a, b, |_, t| ids.extend(t.iter().map(|&v| v as u64 * stride / 4096)));
            ids.sort_unstable();
            ids.dedup();
            pages += ids.len() as u64;
            faces += b - a;
        }
        pages as f64 / faces.max(1) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The packed f32 bounds against a plain loop, for every count of
    /// vertices from 0 to 40 (every remainder of the four-vertex steps),
    /// with a non-finite coordinate planted at every place in turn.
    #[test]
    fn packed_f32_bounds_equal_the_plain_loop_and_refuse_non_finite() {
        let mut state = 7u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 1.0e3
        };
        for n in 0..40usize {
            let coords: Vec<f32> = (0..3 * n).map(|_| next()).collect();
            let bytes: Vec<u8> = coords.iter().flat_map(|c| c.to_le_bytes()).collect();
            let got = packed_f32_bounds(&bytes);
            if n == 0 {
                assert_eq!(got, Some(([f64::INFINITY; 3], [f64::NEG_INFINITY; 3])));
                continue;
            }
            let mut lo = [f64::INFINITY; 3];
            let mut hi = [f64::NEG_INFINITY; 3];
            for (k, &c) in coords.iter().enumerate() {
                lo[k % 3] = lo[k % 3].min(c as f64);
                hi[k % 3] = hi[k % 3].max(c as f64);
            }
            assert_eq!(got, Some((lo, hi)), "{n} vertices");
            for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                for at in 0..3 * n {
                    let mut b = bytes.clone();
                    b[4 * at..4 * at + 4].copy_from_slice(&bad.to_le_bytes());
                    assert_eq!(packed_f32_bounds(&b), None, "{bad} at coordinate {at} of {n} vertices");
                }
            }
        }
    }

    /// A header announcing 2^32 - 1, 2^62 or 2^64 - 1 faces over a file of a
    /// few hundred bytes: the hint stays within the file's size, and reading
    /// reports the truncation (no allocation from the header's count).
    #[test]
    fn lying_face_counts_cap_the_reservation_by_the_file_size() {
        assert_eq!(capacity_hint(u64::MAX, 400, 4), 100);
        assert_eq!(capacity_hint(3, 400, 4), 3);
        assert_eq!(capacity_hint(7, 400, 0), 7);
        let d = tempfile::tempdir().unwrap();
        for n in [u32::MAX as u64, 1u64 << 62, u64::MAX] {
            for (name, el, list) in [("f.ply", "face", "uchar int"), ("s.ply", "tristrips", "int int")] {
                let p = d.path().join(name);
                let mut bytes = format!("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement {el} {n}\nproperty list {list} vertex_indices\nend_header\n").into_bytes();
                for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
                    bytes.extend_from_slice(&v.to_le_bytes());
                }
                if el == "face" {
                    bytes.push(3);
                } else {
                    bytes.extend_from_slice(&3i32.to_le_bytes());
                }
                for i in 0..3i32 {
                    bytes.extend_from_slice(&i.to_le_bytes());
                }
                std::fs::write(&p, &bytes).unwrap();
                let mut r = MeshReader::open(&p, ReadOptions::default()).unwrap();
                assert!(r.face_capacity_hint() as u64 <= bytes.len() as u64 / MIN_FACE_RECORD_BYTES, "{el} {n}");
                let mut chunk = TriangleChunk::new();
                let mut err = None;
                loop {
                    match r.next_chunk(&mut chunk) {
                        Ok(true) => continue,
                        Ok(false) => break,
                        Err(e) => {
                            err = Some(e);
                            break;
                        }
                    }
                }
                let e = err.unwrap_or_else(|| panic!("{el} {n}: no truncation error")).to_string();
                assert!(e.contains("truncated file"), "{e}");
            }
        }
    }
}
